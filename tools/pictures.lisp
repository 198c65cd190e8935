;;;; tools/pictures.lisp -- draw each scene of the page that names the moments of its picture
;;;; (make pictures): report/scene-NAME.svg, shown by the page.

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/workshop")
  (sb-ext:exit :code 2))

(defun physics (name) (find-symbol name '#:luv-physics))

(ensure-directories-exist "report/")
(dolist (scene (symbol-value (physics "*PHYSICS-SCENES*")))
  (let ((name (funcall (physics "PHYSICS-SCENE-NAME") scene))
        (moments (funcall (physics "PHYSICS-SCENE-MOMENTS") scene)))
    (when moments
      (let ((recording (nth-value 1 (funcall (physics "RUN-PHYSICS-SCENE") name :record t)))
            (out (format nil "report/scene-~(~A~).svg" name)))
        (funcall (physics "WRITE-SCENE-PICTURE") recording out moments
                 :title (format nil "~(~A~), " name))
        (format t "~&pictures: ~A (~{~A~^, ~} s)~%" out moments)))))
