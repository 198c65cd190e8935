;;;; tools/pictures.lisp -- draw each standard scene at the moments of its entry (make pictures):
;;;; report/scene-NAME.svg, shown by the page.

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics")
  (sb-ext:exit :code 2))

(ensure-directories-exist "report/")
(dolist (entry (symbol-value (find-symbol "*PHYSICS-SCENES*" '#:luv-physics)))
  (destructuring-bind (name text seconds moments) entry
    (declare (ignore text seconds))
    (let ((recording (nth-value 1 (funcall (find-symbol "RUN-PHYSICS-SCENE" '#:luv-physics) name :record t)))
          (out (format nil "report/scene-~(~A~).svg" name)))
      (funcall (find-symbol "WRITE-SCENE-PICTURE" '#:luv-physics) recording out moments
               :title (format nil "~(~A~), " name))
      (format t "~&pictures: ~A (~{~A~^, ~} s)~%" out moments))))
