;;;; tools/demo.lisp -- load luv-physics and run a scene of the page (make demo, SCENE=basin by
;;;; default: the main job).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/workshop")
  (sb-ext:exit :code 2))

(let ((run (find-symbol "RUN-DEFAULT-SCENE" '#:luv-physics))
      (scene (intern (string-upcase (or (sb-ext:posix-getenv "SCENE") "basin")) :keyword)))
  (handler-case
      (let ((world (funcall run :scene scene))
            (save (sb-ext:posix-getenv "SAVE")))
        ;; SAVE=file writes the world as the scene left it (#SNDISK); make view FILE= can show it
        (when (and save (string/= save ""))
          (format t "~&demo: wrote ~D bytes to ~A~%"
                  (funcall (find-symbol "WRITE-PHYSICS-WORLD" '#:luv-physics) world save) save)))
    (error (e)
      (format *error-output* "demo: ~A~%" e)
      (sb-ext:exit :code 1))))
