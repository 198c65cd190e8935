;;;; tools/api-index.lisp -- write report/api-index.org, the index of the exported symbols that
;;;; physics.html includes, from the loaded image (make html).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/workshop")
  (sb-ext:exit :code 2))

(ensure-directories-exist "report/")
(format t "~&html: report/api-index.org, ~D exported symbols~%"
        (funcall (find-symbol "WRITE-API-INDEX" '#:luv-physics) "report/api-index.org"))
